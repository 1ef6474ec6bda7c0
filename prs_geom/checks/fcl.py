"""Verification of the analytic contact distances with python-fcl (docs/theory/contact.md).

For each side (screw-roller, roller-nut) a fine mesh patch of each flank is built once
around the analytic nearest point of a reference contact, in the part's own frame, with
half the verification's chordal tolerance each (so the two patches together move the
distance by at most that tolerance). FCL's BVH of each patch is then *moved with
transforms* to every checked contact (several rollers and teeth): a rotation about the
part axis that takes the reference nearest point to the contact's nearest point, plus the
axial shift of the helix (the warp at the contact, without the profile term, so the moved
patch stays on the thread surface). For a constant-pitch part the moved patch lies exactly
on the surface; for a graded part the error is the change of warp slope across the patch,
~|c'(m_i) - c'(m_0)| * patch half-length, listed as ``transform_error_bound_mm``. The
patches cover the radii of every contact's nearest point plus a margin (at least
``PATCH_HALF_SIZE_MM``); when FCL's nearest point lands on an artificial patch edge the
margin is doubled and the side measured again.

Each roller is *settled* axially so that its closest checked contact has the axial
clearance ``VERIFY_CLEARANCE_MM`` (FCL's distance is zero for touching or overlapping
meshes): a rigid shift per roller, so tooth-to-tooth differences (graded pitch) stay
visible. One shift for all rollers would leave rollers that do not mesh alike (non-standard
sizing) up to half a pitch apart, where the nearest points wander millimetres off the
contact.

Verdict: the FCL distance and the analytic Euclidean distance (common normal,
:func:`prs_geom.contact.euclidean_distance`) must agree within
``difference_tolerance_mm`` = patch chord tolerance + the transform error bound. Every
comparison beyond it is listed in ``warnings`` (side, roller, tooth, both distances, the
difference and the tolerance), with the likely reason: an analytic nearest point outside
the real flank (between root and crest radius; the analytic surfaces continue beyond the
truncation, so such a "contact" is really an edge contact the analytic model does not
describe), or an FCL nearest point still on a patch edge.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import fcl
import numpy as np
from numpy.typing import NDArray

from prs_geom.analysis.contact import euclidean_distance, solve_collinear, theoretical_screw, tooth_contacts
from prs_geom.geometry.profiles import ThreadProfile
from prs_geom.model.design import PRSDesign

#: Axial clearance (mm) each roller is settled to at its closest checked contact.
VERIFY_CLEARANCE_MM = 0.005
#: Smallest patch margin (mm) around the analytic nearest points.
PATCH_HALF_SIZE_MM = 0.35
#: Patch margin growths (x2 each) allowed when FCL's nearest point sits on a patch edge.
MAX_PATCH_GROWTH = 3
#: A nearest point closer than this many grid steps to an artificial patch edge counts as on it.
EDGE_STEPS = 1.0
#: Analytic points this far (mm) outside the flank's radial band count as off the flank.
BAND_SLACK_MM = 1e-9


def _grid_mesh(u: NDArray, v: NDArray, fn) -> tuple[NDArray, NDArray]:
    """Triangulated parameter grid u x v mapped by fn(U, V) -> (n, 3)."""
    U, V = np.meshgrid(u, v, indexing="ij")
    P = fn(U.ravel(), V.ravel())
    nu, nv = len(u), len(v)
    idx = np.arange(nu * nv).reshape(nu, nv)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return P, F


def patch_radii(part, r_values: NDArray | float, half: float) -> tuple[float, float]:
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


def _patch_kappa(prof) -> float:
    """A bound of the normal curvature (1/mm) of a flank surface."""
    kappa = 2.0 / prof.inner_radius
    kappa = max(kappa, prof.flank.curvature_bound(prof.outer_radius))
    return kappa


def patch_step(part, tol: float) -> float:
    """Grid step (mm) of a patch with chordal error <= tol (see :func:`flank_patch`)."""
    return math.sqrt(4.0 * tol / _patch_kappa(part.profile))


def flank_patch(part, r_c: float, th_c: float, m: float, xi: float, tol: float,
                half: float = PATCH_HALF_SIZE_MM,
                r_range: tuple[float, float] | None = None) -> tuple[NDArray, NDArray, float]:
    """Patch of Z(r, theta) around (r_c, th_c) in the part frame with chordal error <= tol.

    Radii ``r_range`` (default r_c +- half clipped to the flank, :func:`patch_radii`),
    angles th_c +- half / r_c. Grid step h from the sagitta bound: a cell diagonal of
    length sqrt(2) h sags by at most 2 h^2 kappa / 8 = tol (kappa a bound of the normal
    curvature); the achieved error is measured at the triangle centroids and returned.
    """
    h = patch_step(part, tol)
    r_lo, r_hi = r_range if r_range is not None else patch_radii(part, r_c, half)
    nr = max(2, int(math.ceil((r_hi - r_lo) / h)) + 1)
    nt = max(2, int(math.ceil(2 * half / h)) + 1)
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
    Zs, slope = part.z_derivatives(rc, tc, np.full_like(rc, m), np.full_like(rc, xi))[:2]
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

    @property
    def difference_mm(self) -> float:
        return self.fcl_distance_mm - self.analytic_distance_mm

    def as_dict(self) -> dict[str, Any]:
        d = dict(self.__dict__)
        d["difference_mm"] = self.difference_mm
        return d


@dataclass
class _Patch:
    """A flank patch in its part frame and the data to tell its artificial edges."""

    obj: fcl.CollisionObject
    r_lo: float
    r_hi: float
    r_edge_real: tuple[bool, bool]   # r_lo / r_hi is the real root or crest radius
    th_c: float
    half_angle: float
    step: float
    error: float
    triangles: int

    def on_artificial_edge(self, p_local: NDArray) -> bool:
        """Whether a point (patch frame) lies on an edge the flank does not have."""
        r = math.hypot(p_local[0], p_local[1])
        dth = math.atan2(-p_local[0] * math.sin(self.th_c) + p_local[1] * math.cos(self.th_c),
                         p_local[0] * math.cos(self.th_c) + p_local[1] * math.sin(self.th_c))
        e = EDGE_STEPS * self.step
        if not self.r_edge_real[0] and r <= self.r_lo + e:
            return True
        if not self.r_edge_real[1] and r >= self.r_hi - e:
            return True
        return abs(dth) >= self.half_angle - e / r     # the angular edges are always artificial


def _build_patch(part, r_pts: NDArray, r_c: float, th_c: float, m: float, xi: float, tol: float,
                 half: float) -> _Patch:
    lo, hi = patch_radii(part, r_pts, half)
    V, F, err = flank_patch(part, r_c, th_c, m, xi, tol, half, (lo, hi))
    prof = part.profile
    real = (abs(lo - prof.inner_radius) <= 1e-12 * hi, abs(hi - prof.outer_radius) <= 1e-12 * hi)
    return _Patch(fcl.CollisionObject(bvh_model(V, F), fcl.Transform()), lo, hi, real, th_c,
                  half / r_c, patch_step(part, tol), err, int(len(F)))


def _helix_z(part, m: NDArray, th: NDArray) -> NDArray:
    """Axial position W(m + L theta / 2 pi) of the tooth mid-plane (no profile term)."""
    return part.warp(m + part.profile.lead * th / (2 * math.pi))


def _off_band(part, r: float) -> bool:
    prof = part.profile
    return r < prof.inner_radius - BAND_SLACK_MM or r > prof.outer_radius + BAND_SLACK_MM


def verify_side(design: PRSDesign, side: str, tol: float, rollers: NDArray, teeth: NDArray,
                screw_profile=None) -> tuple[list[Comparison], dict[str, float], list[str]]:
    """FCL vs analytic distances for one side (upper flank contacts).

    Returns the comparisons, the patch data (the ``patches`` entry of the report) and one
    note per comparison (empty, or why its difference may be large).
    """
    batch, q0, info = tooth_contacts(design, side, "upper", rollers, teeth, screw_profile)
    first = solve_collinear(batch, q0)
    # settle each roller (rigid axial shift) to VERIFY_CLEARANCE_MM at its closest contact
    shift = np.empty(batch.n)
    for k in np.unique(info["roller"]):
        sel = info["roller"] == k
        shift[sel] = VERIFY_CLEARANCE_MM - float(first.gap[sel].min())
    batch.z_offset[:] = -batch.xi_b * shift        # positive shift opens the gap
    sol = solve_collinear(batch, first.q)
    dist, q = euclidean_distance(batch, sol.q)
    pa, pb = batch.points(q)
    A, B = batch.A, batch.B
    # reference = contact 0; every contact's nearest point maps onto the reference angle
    ra, tha, rb, phb = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    hA = _helix_z(A, batch.m_a, tha)
    hB = _helix_z(B, batch.m_b, phb)
    notes: list[list[str]] = [[] for _ in range(batch.n)]
    for i in range(batch.n):
        off = [f"{name} r = {r:.4f} mm outside its flank {part.profile.inner_radius:.4f}-"
               f"{part.profile.outer_radius:.4f} mm"
               for name, part, r in ((side, A, ra[i]), ("roller", B, rb[i])) if _off_band(part, r)]
        if off:
            notes[i].append("the analytic nearest point lies off the real flank (" + "; ".join(off)
                            + "): the analytic surfaces continue beyond root and crest, so this is "
                            "an edge contact the analytic model does not describe")
    half = PATCH_HALF_SIZE_MM
    for growth in range(MAX_PATCH_GROWTH + 1):
        pA = _build_patch(A, ra, ra[0], tha[0], batch.m_a[0], batch.xi_a[0], 0.5 * tol, half)
        pB = _build_patch(B, rb, rb[0], phb[0], batch.m_b[0], batch.xi_b[0], 0.5 * tol, half)
        out, on_edge = [], np.zeros(batch.n, bool)
        for i in range(batch.n):
            RA = _rot_z(tha[i] - tha[0])
            tA = np.array([0.0, 0.0, hA[i] - hA[0]])
            pA.obj.setTransform(fcl.Transform(RA, tA))
            RB = _rot_z(batch.alpha[i]) @ _rot_z(phb[i] - phb[0])
            tB = np.array([batch.ox[i], batch.oy[i], hB[i] - hB[0] + batch.z_offset[i]])
            pB.obj.setTransform(fcl.Transform(RB, tB))
            req = fcl.DistanceRequest(enable_nearest_points=True)
            res = fcl.DistanceResult()
            d_fcl = fcl.distance(pA.obj, pB.obj, req, res)
            npts = np.array(res.nearest_points)
            pdiff = max(np.linalg.norm(npts[0] - pa[i]), np.linalg.norm(npts[1] - pb[i]))
            # touching or overlapping patches have no meaningful nearest points
            on_edge[i] = d_fcl > 0 and (pA.on_artificial_edge(RA.T @ (npts[0] - tA))
                                        or pB.on_artificial_edge(RB.T @ (npts[1] - tB)))
            out.append(Comparison(side, int(info["roller"][i]), int(info["tooth"][i]), float(dist[i]),
                                  float(d_fcl), float(pdiff)))
        if not on_edge.any():
            break
        if growth < MAX_PATCH_GROWTH:
            half *= 2.0
    for i in np.flatnonzero(on_edge):
        notes[i].append(f"FCL's nearest point lies on an edge of the {2 * half:.3g} mm patch")
    slope_err = 0.0
    for part, m_arr, th_arr, r_arr in ((A, batch.m_a, tha, ra), (B, batch.m_b, phb, rb)):
        k = part.profile.lead / (2 * math.pi)
        s = part.warp.correction_slope(m_arr + k * th_arr)
        # the patch spans +- half / r_arr[0] in angle, i.e. +- k half / r_arr[0] in the warp argument
        slope_err = max(slope_err, float(np.max(np.abs(s - s[0]))) * k * half / float(r_arr[0]))
    meta = {"patch_error_mm": max(pA.error, pB.error), "patch_triangles": pA.triangles + pB.triangles,
            "axial_separation_mm": float(np.max(np.abs(shift))), "transform_error_bound_mm": slope_err}
    return out, meta, ["; ".join(n) for n in notes]


def comparison_warning(c: Comparison, tolerance: float, note: str = "") -> str:
    """One line naming the comparison, both distances, the difference and the tolerance."""
    pair = "screw-roller" if c.side == "screw" else "roller-nut"
    msg = (f"{pair} contact, roller {c.roller}, tooth {c.tooth}: FCL distance "
           f"{c.fcl_distance_mm:.6f} mm vs analytic distance {c.analytic_distance_mm:.6f} mm, "
           f"difference {c.difference_mm:+.3g} mm exceeds the tolerance {tolerance:.3g} mm")
    return msg + (f" ({note})" if note else "")


def check_comparisons(comps: list[Comparison], tolerance: float,
                      notes: list[str] | None = None) -> list[str]:
    """Warnings for every comparison whose |FCL - analytic| exceeds ``tolerance`` (mm)."""
    notes = notes or [""] * len(comps)
    return [comparison_warning(c, tolerance, n) for c, n in zip(comps, notes)
            if not abs(c.difference_mm) <= tolerance]


def verify_contacts(design: PRSDesign, tol: float = 0.001,
                    screw_profile: ThreadProfile | None = None) -> dict[str, Any]:
    """``checks.fcl`` of the report: FCL vs analytic on both sides, with the theoretical
    screw ``screw_profile`` of the contact stage (solved here when not given).

    ``difference_tolerance_mm`` = ``tol`` (each of the two patches is built for tol / 2)
    + the larger transform error bound of the two sides; ``warnings`` lists every
    comparison whose |FCL - analytic| exceeds it (empty when all agree).
    """
    t0 = time.perf_counter()
    z, n = design.roller.count, design.thread.engaged_teeth
    rollers = np.unique([0, z // 3, (2 * z) // 3])
    teeth = np.unique([1, (n + 1) // 2, n])
    if screw_profile is None:
        screw_profile = theoretical_screw(design).profile
    comps, meta, notes = [], {}, []
    for side in ("screw", "nut"):
        c, m, nt = verify_side(design, side, tol, rollers, teeth, screw_profile)
        comps += c
        notes += nt
        meta[side] = m
    tolerance = tol + max(m["transform_error_bound_mm"] for m in meta.values())
    diffs = [abs(c.difference_mm) for c in comps]
    return {
        "patch_chord_tolerance_mm": tol,
        "difference_tolerance_mm": tolerance,
        "comparisons": [c.as_dict() for c in comps],
        "max_abs_difference_mm": float(max(diffs)),
        "max_point_difference_mm": float(max(c.point_difference_mm for c in comps)),
        "patches": meta,
        "warnings": check_comparisons(comps, tolerance, notes),
        "time_s": time.perf_counter() - t0,
    }
